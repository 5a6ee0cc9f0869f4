// Validates YAML job files against a JSON Schema with ajv (the test test_job_schema runs it):
//   node validate_jobs.mjs SCHEMA.json JOB.yaml ...
// One JSON line per job on stdout: {"file", "valid", "errors": [ajv's errors]}.
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const web = process.env.SCANPLAN_WEB_MODULES;  // web/node_modules
const Ajv = require(`${web}/ajv`).default ?? require(`${web}/ajv`);
const YAML = require(`${web}/yaml`);

const [schemaFile, ...jobs] = process.argv.slice(2);
const ajv = new Ajv({ allErrors: true, strict: true, allowUnionTypes: true });
const validate = ajv.compile(JSON.parse(readFileSync(schemaFile, 'utf8')));
for (const file of jobs) {
  const valid = validate(YAML.parse(readFileSync(file, 'utf8')));
  console.log(JSON.stringify({ file, valid, errors: validate.errors ?? [] }));
}
